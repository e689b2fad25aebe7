//! The `mra` command line. A thin `clap` shell: every command calls the library and
//! adds the file name to errors. One file per command group.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

pub mod analyze;
pub mod array;
pub mod codec;
pub mod curve;
pub mod demo;
pub mod denoise;
pub mod io_cmds;
pub mod label;
pub mod mesh;
pub mod outputs;
pub mod points;
pub mod scheme;
#[cfg(feature = "serve")]
pub mod serve;
pub mod solid;
pub mod stdio;
pub mod style;
pub mod subdivide;
pub mod surface;
pub mod terrain;
pub mod transfer;
pub mod upscale;

/// Multiresolution codec, upscaler and terrain synthesis for images, volumes and heightmaps.
#[derive(Parser, Debug)]
#[command(
    name = "mra",
    version,
    about,
    long_about = None,
    after_help = "Environment:\n  MRA_MAX_BYTES  memory budget for one raster, decoded or planned (default 8G; e.g. 512M, 32G):\n                 a file whose header declares more, or a command whose output would take\n                 more, is refused before anything is allocated"
)]
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
    /// The old name of `info` (kept for scripts).
    #[command(hide = true)]
    InfoFile(io_cmds::InfoFileArgs),
    /// Convert between image / volume / heightmap formats, keeping samples exact.
    Convert(io_cmds::ConvertArgs),
    /// Schemes: which MRA scheme keeps your image best (`keep`), eigen-analysis of a
    /// subdivision mask (`analyze`).
    #[command(subcommand)]
    Scheme(scheme::Command),
    /// Terrain: synthesis by example (§9.7.4), hillshaded rendering.
    #[command(subcommand)]
    Terrain(terrain::TerrainCommand),
    /// Give an image, heightmap or volume the fine details of an example (detail transfer).
    Transfer(transfer::TransferArgs),
    /// Remove noise by thresholded details (§9.7.2): curves, images, volumes, heightmaps.
    Denoise(denoise::DenoiseArgs),

    /// Upscale images, volumes, heightmaps by subdivision / B-spline interpolation (§7.7).
    Upscale(upscale::UpscaleArgs),
    /// Reduce resolution with the MRA's analysis filter A (REDUCE-RESOLUTION, §9).
    Downscale(upscale::DownscaleArgs),
    /// Compress an image / volume / heightmap into an .mra file.
    Encode(codec::EncodeArgs),
    /// Decompress an .mra file (optionally at reduced resolution).
    Decode(codec::DecodeArgs),
    /// Show what a file holds: format, shape, sample type, range, metadata (x, y, z
    /// order); for an .mra file its header and bytes per level.
    Info(io_cmds::InfoFileArgs),
    /// Solid modelling: implicit models, CSG, ray casting, polygonisation, voxelisation.
    #[command(subcommand)]
    Solid(solid::Command),
    /// Volumes: isosurfaces of CT/MR data.
    #[command(subcommand)]
    Volume(solid::VolumeCommand),
    /// Serve the .mra files of a folder over HTTP: IIIF Image API 3.0 and a deep-zoom viewer.
    #[cfg(feature = "serve")]
    Serve(serve::ServeArgs),
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

/// The longest error message printed; the rest is counted, not shown (a message may quote
/// bytes of a damaged file).
pub const MAX_MESSAGE_CHARS: usize = 400;

/// `message` as one printable line: control characters (newlines, tabs, escapes) become
/// spaces, runs of spaces one space, undecodable bytes `?`, and past
/// [`MAX_MESSAGE_CHARS`] the text is cut with "… (N more characters)".
pub fn one_line(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(MAX_MESSAGE_CHARS + 32));
    let mut shown = 0usize;
    let mut hidden = 0usize;
    let mut space = false;
    for c in message.trim().chars() {
        let c = match c {
            c if c.is_control() || c.is_whitespace() => ' ',
            '\u{FFFD}' => '?',
            c => c,
        };
        if c == ' ' {
            if space {
                continue;
            }
            space = true;
        } else {
            space = false;
        }
        if shown < MAX_MESSAGE_CHARS {
            out.push(c);
            shown += 1;
        } else {
            hidden += 1;
        }
    }
    if hidden > 0 {
        out.push_str(&format!("… ({hidden} more characters)"));
    }
    out
}

/// The clap command of `mra`, with the conventions every subcommand shares: a value that
/// reads as a negative number (`--bpp -1`) is taken as the option's value, so that its
/// check can name it invalid (instead of clap calling it an unexpected argument).
pub fn command() -> clap::Command {
    fn negatives(c: clap::Command) -> clap::Command {
        c.mut_args(|a| {
            if a.get_action().takes_values() {
                a.allow_negative_numbers(true)
            } else {
                a
            }
        })
        .mut_subcommands(negatives)
    }
    negatives(Cli::command())
}

/// A clap error as one line: its first paragraph (the message, and for missing arguments
/// the names of the missing ones), without the usage and the tips.
fn clap_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let first: Vec<&str> = text
        .lines()
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| !l.trim().is_empty())
        .map(|l| l.trim())
        .collect();
    let msg = first.join(" ");
    let msg = msg.trim_start_matches("error: ");
    if msg.is_empty() {
        "invalid arguments".into()
    } else {
        one_line(msg)
    }
}

/// Parse the arguments, run the command, and return the process exit code: 0 on success,
/// 2 with one line on stderr on any failure (bad arguments included), and 2 with the help
/// on stderr when a command is missing (`mra` alone, `mra curve`).
pub fn main() -> i32 {
    let parsed = command().try_get_matches().and_then(|m| {
        let name = m.subcommand_name().unwrap_or("mra").to_string();
        Cli::from_arg_matches(&m).map(|cli| (cli, name))
    });
    let (cli, name) = match parsed {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind as K;
            return match e.kind() {
                K::DisplayHelp | K::DisplayVersion => {
                    let _ = e.print();
                    0
                }
                K::DisplayHelpOnMissingArgumentOrSubcommand => {
                    eprint!("{}", e.render());
                    2
                }
                _ => {
                    eprintln!("mra: {}", clap_line(&e));
                    2
                }
            };
        }
    };
    let args: Vec<std::ffi::OsString> = std::env::args_os().skip(1).collect();
    if let Err(f) = outputs::check(&args) {
        eprintln!("mra: {f}");
        return 2;
    }
    // `--quiet` of any command also hides the command's spinner
    let quiet = args.iter().any(|a| a == "--quiet");
    let activity = crate::progress::Activity::start(&name, quiet);
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
        Command::InfoFile(a) => info(a),
        Command::Convert(a) => io_cmds::convert(a),
        Command::Scheme(c) => scheme::run(c),
        Command::Terrain(c) => terrain::run(c),
        Command::Transfer(a) => transfer::transfer(a),
        Command::Denoise(a) => denoise::denoise(a),
        Command::Upscale(a) => upscale::run_upscale(a),
        Command::Downscale(a) => upscale::run_downscale(a),
        Command::Encode(a) => codec::encode(a),
        Command::Decode(a) => codec::decode(a),
        Command::Info(a) => info(a),
        Command::Solid(c) => solid::run(c),
        Command::Volume(c) => solid::run_volume(c),
        #[cfg(feature = "serve")]
        Command::Serve(a) => serve::run(a),
    };
    drop(activity);
    match result {
        Ok(()) => 0,
        Err(f) => {
            eprintln!("mra: {}", one_line(&f.to_string()));
            2
        }
    }
}

/// `mra info` (and its old name `info-file`): `.mra` files by their header, anything else
/// by reading it (here, above both commands' files, so neither imports the other).
fn info(a: io_cmds::InfoFileArgs) -> CliResult {
    if a.raw.dims.is_none() && io_cmds::is_std(&a.input) {
        // standard input is read once, then told apart by its signature
        let bytes = io_cmds::stdin_bytes()?;
        if bytes.starts_with(&crate::format::SIGNATURE) {
            return codec::info_bytes("standard input", &bytes, a.json);
        }
        return io_cmds::info_file(a, Some(bytes));
    }
    if a.raw.dims.is_none() && io_cmds::is_mra(&a.input) {
        return codec::info(codec::InfoArgs {
            input: a.input,
            json: a.json,
        });
    }
    io_cmds::info_file(a, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_become_one_printable_bounded_line() {
        assert_eq!(one_line("a\nb\r\n\tc  d"), "a b c d");
        assert_eq!(one_line("bad \u{1b}[31m\u{0}x\u{FFFD}"), "bad [31m x?");
        let long = "x".repeat(MAX_MESSAGE_CHARS + 50);
        let l = one_line(&long);
        assert!(l.starts_with(&"x".repeat(MAX_MESSAGE_CHARS)));
        assert!(l.ends_with("… (50 more characters)"), "{l}");
    }

    #[test]
    fn the_command_is_consistent() {
        command().debug_assert();
    }
}
