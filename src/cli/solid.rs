//! `mra solid …` (implicit models and CSG scenes) and `mra volume isosurface` (surfaces out of
//! CT/MR volumes). A thin shell over `crate::solid`.

use super::mesh::MeshOut;
use super::{stdio, CliResult, Failure};
use crate::solid::{mc, render, scene::Scene, tlist, voxel};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Ray-cast a scene (CSG t-lists, exact spheres, root finding for the rest) to PNG.
    ///
    /// Example: mra solid render corpus/scenes/csg20.json -o csg.png --size 512
    Render {
        #[command(flatten)]
        scene: SceneFile,
        /// Output PNG (`-`: standard output).
        #[arg(short, long)]
        output: PathBuf,
        /// Image width and height in pixels.
        #[arg(long, default_value_t = 512)]
        size: usize,
    },
    /// Sample a scene on a grid and polygonise it by marching cubes (OBJ, PLY or OFF).
    ///
    /// Example: mra solid polygonize corpus/scenes/blend.json -o blend.obj --resolution 128 --normals
    Polygonize {
        #[command(flatten)]
        scene: SceneFile,
        #[command(flatten)]
        out: MeshOut,
        /// Cells along the longest side of the model.
        #[arg(long, default_value_t = 128)]
        resolution: usize,
        /// Write vertex normals from the field's gradient.
        #[arg(long)]
        normals: bool,
    },
    /// Write a scene as a volume (NRRD, NIfTI, raw, TIFF by extension): the field F as
    /// float32, or occupancy as uint8 (255 inside).
    ///
    /// Example: mra solid voxelize corpus/scenes/box_minus_cylinder.json -o part.nrrd --size 128 --occupancy
    Voxelize {
        #[command(flatten)]
        scene: SceneFile,
        /// Output volume: NRRD, NIfTI, raw or TIFF, by extension (`-`: standard output, with
        /// --format).
        #[arg(short, long)]
        output: PathBuf,
        /// Format of `-o -` (standard output): nrrd, nii, tif or raw.
        #[arg(long, value_name = "EXT")]
        format: Option<String>,
        /// Cells along the longest side of the model.
        #[arg(long, default_value_t = 128)]
        size: usize,
        /// Store 255 inside / 0 outside instead of the field.
        #[arg(long)]
        occupancy: bool,
    },
    /// Volume of a scene's solid from the t-lists of parallel rays.
    ///
    /// Example: mra solid volume corpus/scenes/sphere_and_box.json --rays 512
    Volume {
        #[command(flatten)]
        scene: SceneFile,
        /// Rays per side of the grid of parallel rays (1 to 16384).
        #[arg(long, default_value_t = tlist::DEFAULT_RAYS, value_parser = parse_rays)]
        rays: usize,
    },
}

/// The scene a solid command reads.
#[derive(Args, Debug)]
pub struct SceneFile {
    /// Scene file (JSON: primitives, CSG operations, blends; examples in corpus/scenes;
    /// `-`: standard input).
    scene: PathBuf,
}

/// Most rays per side of `solid volume` (16384² ≈ 2.7 × 10⁸ rays).
pub const MAX_RAYS: usize = 1 << 14;

fn parse_rays(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_RAYS).contains(&n) => Ok(n),
        _ => Err(format!("{s} rays per side (expected 1 to {MAX_RAYS})")),
    }
}

/// `mra volume …`.
#[derive(Subcommand, Debug)]
pub enum VolumeCommand {
    /// Extract the isosurface `value = level` of a volume (NRRD, NIfTI, DICOM folder, raw,
    /// TIFF stack) as a closed, manifold triangle mesh in physical units (mm with the file's
    /// spacing). The volume border is capped so surfaces leaving the volume are closed.
    ///
    /// Example: mra volume isosurface CT.nrrd --level 300 -o bone.obj
    Isosurface(IsoArgs),
}

#[derive(Args, Debug)]
pub struct IsoArgs {
    /// A volume (any format `mra info-file` reads: NRRD, NIfTI, DICOM folder, TIFF stack, raw).
    pub input: PathBuf,
    #[command(flatten)]
    pub out: MeshOut,
    /// Iso value (inside is above it).
    #[arg(long)]
    pub level: f64,
    /// Do not cap the volume border (surfaces touching it stay open, as in scikit-image).
    #[arg(long)]
    pub open: bool,
    /// Write vertex normals from the volume's gradient.
    #[arg(long)]
    pub normals: bool,
    /// Also check the mesh's topology (closed, manifold, oriented, Euler characteristic χ);
    /// about as long as the marching cubes on a large surface.
    #[arg(long)]
    pub check: bool,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write PLY positions as `double` (default `float`, as scikit-image and VTK).
    #[arg(long)]
    pub double: bool,
}

fn scene(path: &Path) -> Result<Scene, Failure> {
    stdio::input(
        path,
        |_| "json",
        |p| Scene::read(p).map_err(|e| Failure::context(p.display(), e)),
    )
}

fn write_mesh(path: &Path, format: Option<&str>, iso: mc::Isosurface) -> CliResult {
    write_mesh_as(path, format, iso, None)
}

/// [`write_mesh`] with the PLY position type (`float` for volume isosurfaces, as
/// scikit-image and VTK write them; `double` by default).
fn write_mesh_as(
    path: &Path,
    format: Option<&str>,
    iso: mc::Isosurface,
    position: Option<crate::mesh::attributes::ScalarType>,
) -> CliResult {
    let mut m = iso.mesh;
    m.attributes.position_type = position;
    m.attributes.vertex_normals = iso.normals;
    stdio::output(path, format, None, "obj, ply, off", |p| {
        crate::mesh::io::write(p, &m).map_err(|e| Failure::context(p.display(), e))
    })
}

/// Print what was made: counts, area, enclosed volume and time; with `check`, the
/// topology too (closed, manifold, oriented, χ); as text or one JSON object.
/// On standard error when `output` is standard output.
fn report(output: &Path, iso: &mc::Isosurface, secs: f64, check: bool, json: bool) -> CliResult {
    let topo = check.then(|| crate::mesh::topology::analyze(&iso.mesh));
    let (area, vol) = mc::area_volume(&iso.mesh);
    let (nv, nf) = (iso.mesh.vertex_count(), iso.mesh.face_count());
    let text = if json {
        let v = serde_json::json!({
            "vertices": nv,
            "triangles": nf,
            "area": area,
            "volume": vol,
            "seconds": secs,
            "closed": topo.as_ref().map(|r| r.closed),
            "manifold": topo.as_ref().map(|r| r.manifold),
            "oriented": topo.as_ref().map(|r| r.oriented),
            "euler": topo.as_ref().map(|r| r.euler),
        });
        v.to_string()
    } else {
        let t = topo
            .map(|r| {
                format!(
                    ", closed {}, manifold {}, oriented {}, χ {}",
                    r.closed, r.manifold, r.oriented, r.euler
                )
            })
            .unwrap_or_default();
        format!("{nv} vertices, {nf} triangles{t}, area {area:.6}, volume {vol:.6}, {secs:.3} s")
    };
    super::io_cmds::report(output, &text)
}

pub fn run(c: Command) -> CliResult {
    match c {
        Command::Render {
            scene: s,
            output,
            size,
        } => {
            let sc = scene(&s.scene)?;
            let t = Instant::now();
            let img = render::render(&sc, size, size)?;
            let secs = t.elapsed().as_secs_f64();
            let bytes = render::png_bytes(&img)?;
            stdio::write_bytes(&output, &bytes)?;
            super::io_cmds::report(
                &output,
                &format!(
                    "{}x{} image of {} primitives in {:.3} s",
                    size,
                    size,
                    sc.root.leaf_count(),
                    secs
                ),
            )
        }
        Command::Polygonize {
            scene: s,
            out,
            resolution,
            normals,
        } => {
            let sc = scene(&s.scene)?;
            let t = Instant::now();
            let sampled = voxel::sample(&sc.root, resolution)?;
            let iso = mc::polygonize(&sampled.grid(), 0.0, normals)?;
            report(&out.output, &iso, t.elapsed().as_secs_f64(), true, false)?;
            write_mesh(&out.output, out.format.as_deref(), iso)
        }
        Command::Voxelize {
            scene: s,
            output,
            format,
            size,
            occupancy,
        } => {
            let sc = scene(&s.scene)?;
            let sampled = voxel::sample(&sc.root, size)?;
            let mode = if occupancy {
                voxel::VoxelMode::Occupancy
            } else {
                voxel::VoxelMode::Field
            };
            let r = voxel::to_raster(&sampled, mode)?;
            super::io_cmds::write_output_as(&output, &r, false, None, format.as_deref())?;
            super::io_cmds::report(
                &output,
                &format!(
                    "{} x {} x {} samples, spacing {:.6}",
                    sampled.dims[0], sampled.dims[1], sampled.dims[2], sampled.spacing[0]
                ),
            )
        }
        Command::Volume { scene: s, rays } => {
            let sc = scene(&s.scene)?;
            let t = Instant::now();
            let bar = crate::progress::Progress::new(rays as u64, "rays", false);
            let v = tlist::volume_with(&sc.root, rays, tlist::DEFAULT_STEPS, &bar)?;
            bar.finish();
            println!(
                "volume {v:.9} ({rays}x{rays} rays, {:.3} s)",
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
    }
}

/// Samples (x fastest), dims `[nx, ny, nz]`, spacing and origin (x, y, z) of a volume grid.
pub type VolumeGrid = (Vec<f32>, [usize; 3], [f64; 3], [f64; 3]);

/// The volume as a grid (x fastest, physical spacing), optionally padded by one sample of
/// `−∞`-like value on every side so the isosurface closes at the border.
pub fn volume_grid(r: &crate::io::Raster, cap: bool) -> Result<VolumeGrid, Failure> {
    into_volume_grid(r.clone(), cap)
}

/// [`volume_grid`] taking the raster: `f32` samples are used in place (no copy), and the
/// padding grows that same buffer, so a 256³ volume costs no second 64 MiB array (whose
/// fresh pages the kernel must clear: a fifth of the whole `volume isosurface` on the
/// peer benchmark).
pub fn into_volume_grid(r: crate::io::Raster, cap: bool) -> Result<VolumeGrid, Failure> {
    if r.channels != 1 || r.dims.len() != 3 {
        return Err(Failure(format!(
            "volume with dims {:?} and {} channels (expected a single-channel 3-D volume)",
            r.dims, r.channels
        )));
    }
    let (nz, ny, nx) = (r.dims[0], r.dims[1], r.dims[2]);
    let sp = r
        .meta
        .spacing
        .clone()
        .filter(|s| s.len() == 3)
        .unwrap_or(vec![1.0; 3]);
    let spacing = [sp[2], sp[1], sp[0]];
    let origin = r
        .meta
        .origin
        .clone()
        .filter(|o| o.len() == 3)
        .map(|o| [o[0], o[1], o[2]])
        .unwrap_or([0.0; 3]);
    let mut v = match r.samples {
        crate::io::Samples::F32(v) => v,
        other => other.to_f32(),
    };
    if !cap {
        return Ok((v, [nx, ny, nz], spacing, origin));
    }
    let low = v.iter().copied().fold(f32::INFINITY, f32::min);
    let pad = if low.is_finite() {
        low - 1.0 - low.abs()
    } else {
        -1.0
    };
    let (px, py, pz) = (nx + 2, ny + 2, nz + 2);
    crate::limits::Limits::from_env()?.check_elems(
        "padded volume samples (memory budget MRA_MAX_BYTES)",
        (px * py) as u64 * pz as u64,
        4,
    )?;
    v.resize(px * py * pz, pad);
    // row (j, k) moves from (k·ny + j)·nx to ((k+1)·py + j+1)·px + 1, never to an earlier
    // place: moved last row first, no row overwrites one not yet moved
    for k in (0..nz).rev() {
        for j in (0..ny).rev() {
            let src = (k * ny + j) * nx;
            let dst = ((k + 1) * py + j + 1) * px + 1;
            v.copy_within(src..src + nx, dst);
        }
    }
    // the border: plane 0, and in each inner plane rows 0 and py−1 and the two end
    // samples of every row (plane pz−1 came from `resize` or is overwritten below)
    v[..px * py].fill(pad);
    for k in 1..=nz {
        let plane = &mut v[k * px * py..(k + 1) * px * py];
        plane[..px].fill(pad);
        plane[(py - 1) * px..].fill(pad);
        for j in 1..=ny {
            plane[j * px] = pad;
            plane[j * px + px - 1] = pad;
        }
    }
    v[(pz - 1) * px * py..].fill(pad);
    let origin = [
        origin[0] - spacing[0],
        origin[1] - spacing[1],
        origin[2] - spacing[2],
    ];
    Ok((v, [px, py, pz], spacing, origin))
}

pub fn run_volume(c: VolumeCommand) -> CliResult {
    match c {
        VolumeCommand::Isosurface(a) => {
            crate::tuning::use_allocator(crate::tuning::Allocator::ReuseFreed);
            let r = super::io_cmds::read_input(&a.input, &crate::io::ReadOptions::default())?;
            let t = Instant::now();
            let (values, dims, spacing, origin) = into_volume_grid(r, !a.open)?;
            let grid = mc::Grid {
                values: &values,
                dims,
                spacing,
                origin,
            };
            let iso = mc::polygonize(&grid, a.level, a.normals)?;
            drop(values);
            report(
                &a.out.output,
                &iso,
                t.elapsed().as_secs_f64(),
                a.check,
                a.json,
            )?;
            let float = (!a.double).then_some(crate::mesh::attributes::ScalarType::F32);
            write_mesh_as(&a.out.output, a.out.format.as_deref(), iso, float)
        }
    }
}
