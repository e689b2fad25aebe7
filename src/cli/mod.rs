//! The `mra` command line. A thin `clap` shell: every command calls the library and
//! adds the file name to errors. One file per command group.

use clap::{Parser, Subcommand};

pub mod analyze;
pub mod array;
pub mod codec;
pub mod curve;
pub mod demo;
pub mod io_cmds;
pub mod mesh;
pub mod outputs;
pub mod points;
pub mod scheme;
pub mod solid;
pub mod subdivide;
pub mod surface;
pub mod terrain;
pub mod upscale;

/// Multiresolution codec, upscaler and terrain synthesis for images, volumes and heightmaps.
#[derive(Parser, Debug)]
#[command(name = "mra", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run the main jobs on generated data and print what ran, sizes, errors and times.
    Demo(demo::DemoArgs),
    /// Decompose a point list or an array into coarse points and details (§9).
    Analyze(analyze::AnalyzeArgs),
    /// Reconstruct from the output of `analyze`.
    Synthesize(analyze::SynthesizeArgs),
    /// Refine a point list by subdivision (§7).
    Subdivide(subdivide::SubdivideArgs),
    /// Curves: Bézier, B-splines, NURBS (evaluate, split, elevate, insert knots, plot).
    #[command(subcommand)]
    Curve(curve::Command),
    /// Surfaces: patches, lofts, Coons, revolution, sweeps, blends.
    #[command(subcommand)]
    Surface(surface::Command),
    /// Polygon meshes: info, subdivision, smoothing, simplification, rendering.
    #[command(subcommand)]
    Mesh(mesh::Command),
    /// Compare two images / volumes / heightmaps: MSE, PSNR, max error, SSIM.
    Compare(io_cmds::CompareArgs),
    /// Generate test data: zone plate, gradient, edges, strokes, noise, phantom, terrain.
    Generate(io_cmds::GenerateArgs),
    /// Show format, shape, sample type, range and metadata of a file or folder.
    InfoFile(io_cmds::InfoFileArgs),
    /// Convert between image / volume / heightmap formats, keeping samples exact.
    Convert(io_cmds::ConvertArgs),
    /// Curve subdivision schemes: eigen-analysis of a mask.
    #[command(subcommand)]
    Scheme(scheme::Command),
    /// Terrain: synthesis by example (§9.7.4), hillshaded rendering.
    #[command(subcommand)]
    Terrain(terrain::TerrainCommand),
    /// Give an image, heightmap or volume the fine details of an example (detail transfer).
    Transfer(terrain::TransferArgs),
    /// Remove noise by thresholded details (§9.7.2): curves, images, volumes, heightmaps.
    Denoise(terrain::DenoiseArgs),

    /// Upscale images, volumes, heightmaps by subdivision / B-spline interpolation (§7.7).
    Upscale(upscale::UpscaleArgs),
    /// Reduce resolution with the MRA's analysis filter A (REDUCE-RESOLUTION, §9).
    Downscale(upscale::DownscaleArgs),
    /// Compress an image / volume / heightmap into an .mra file.
    Encode(codec::EncodeArgs),
    /// Decompress an .mra file (optionally at reduced resolution).
    Decode(codec::DecodeArgs),
    /// Show an .mra file's header and bytes per level.
    Info(codec::InfoArgs),
    /// Solid modelling: implicit models, CSG, ray casting, polygonisation, voxelisation.
    #[command(subcommand)]
    Solid(solid::Command),
    /// Volumes: isosurfaces of CT/MR data.
    #[command(subcommand)]
    Volume(solid::VolumeCommand),
}

/// A failure on the command line: one line on stderr, exit code 2.
#[derive(Debug)]
pub struct Failure(pub String);

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl From<crate::Error> for Failure {
    fn from(e: crate::Error) -> Self {
        Failure(e.to_string())
    }
}

impl Failure {
    /// Prefix the message with the file (or other context) it concerns.
    pub fn context(what: impl std::fmt::Display, e: impl std::fmt::Display) -> Self {
        Failure(format!("{what}: {e}"))
    }
}

pub type CliResult = std::result::Result<(), Failure>;

/// Parse the arguments, run the command, and return the process exit code.
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind as K;
            let code = match e.kind() {
                K::DisplayHelp
                | K::DisplayVersion
                | K::DisplayHelpOnMissingArgumentOrSubcommand => 0,
                _ => 2,
            };
            if code == 0 {
                let _ = e.print();
            } else {
                // one line: clap's first line of the message
                let msg = e.to_string();
                let first = msg
                    .lines()
                    .find(|l| !l.trim().is_empty())
                    .unwrap_or("invalid arguments");
                eprintln!("mra: {}", first.trim_start_matches("error: "));
            }
            return code;
        }
    };
    let args: Vec<std::ffi::OsString> = std::env::args_os().skip(1).collect();
    if let Err(f) = outputs::check(&args) {
        eprintln!("mra: {f}");
        return 2;
    }
    let result = match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Analyze(a) => analyze::run_analyze(a),
        Command::Synthesize(a) => analyze::run_synthesize(a),
        Command::Subdivide(a) => subdivide::run(a),
        Command::Curve(c) => curve::run(c),
        Command::Surface(c) => surface::run(c),
        Command::Mesh(c) => mesh::run(c),
        Command::Compare(a) => io_cmds::compare(a),
        Command::Generate(a) => io_cmds::generate(a),
        Command::InfoFile(a) => io_cmds::info_file(a),
        Command::Convert(a) => io_cmds::convert(a),
        Command::Scheme(c) => scheme::run(c),
        Command::Terrain(c) => terrain::run(c),
        Command::Transfer(a) => terrain::transfer(a),
        Command::Denoise(a) => terrain::denoise(a),
        Command::Upscale(a) => upscale::run_upscale(a),
        Command::Downscale(a) => upscale::run_downscale(a),
        Command::Encode(a) => codec::encode(a),
        Command::Decode(a) => codec::decode(a),
        Command::Info(a) => codec::info(a),
        Command::Solid(c) => solid::run(c),
        Command::Volume(c) => solid::run_volume(c),
    };
    match result {
        Ok(()) => 0,
        Err(f) => {
            eprintln!("mra: {f}");
            2
        }
    }
}
