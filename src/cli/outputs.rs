//! The one check every command's output path passes before the command runs: the
//! output is never one of the inputs (the same file, also through another path, a
//! symbolic or a hard link), and its extension names what the command writes.
//!
//! It reads the arguments as given: the output is the value of `-o` / `--output`, the
//! inputs every other argument naming an existing file or folder. Commands whose output
//! format is fixed or chosen by the extension are listed in [`expected`].

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use super::Failure;
use crate::io::Format;

/// What a command may write, by its name (`None`: any name its writer accepts).
enum Writes {
    /// Exactly these extensions (lower case, without the dot).
    Extensions(&'static [&'static str]),
    /// A raster format mra writes ([`Format::from_extension`] and writable).
    Raster,
}

/// Point lists (curves, signals): text, one point per line.
const POINTS: &[&str] = &["csv", "txt", "pts", "xy", "xyz"];
/// Meshes: the formats `crate::mesh::io` writes.
const MESHES: &[&str] = &["obj", "ply", "off"];

/// The outputs of the commands whose output kind is known here: `command` and, for a
/// command group (`mesh`, `curve`), its `subcommand`; `input` is the first input named
/// (a point list or a raster for `denoise`).
fn expected(command: &str, subcommand: &str, input: Option<&Path>) -> Option<Writes> {
    Some(match (command, subcommand) {
        ("encode", _) => Writes::Extensions(&["mra"]),
        (
            "decode" | "convert" | "upscale" | "downscale" | "transfer" | "terrain" | "generate",
            _,
        ) => Writes::Raster,
        ("denoise", _) if input.is_some_and(super::stdio::is_std) => return None,
        ("denoise", _) if input.is_some_and(super::analyze::is_point_list) => {
            Writes::Extensions(POINTS)
        }
        ("denoise", _) => Writes::Raster,
        ("mesh", "render") => Writes::Extensions(&["png"]),
        ("mesh", "info" | "analyze") => return None,
        ("mesh", _) => Writes::Extensions(MESHES),
        ("curve", "plot") => Writes::Extensions(&["svg", "png"]),
        ("curve", _) => Writes::Extensions(POINTS),
        _ => return None,
    })
}

/// Raster formats mra writes (the extensions [`crate::io::write`] accepts).
const RASTER_OUT: &str =
    ".png .tif .jpg .pgm .ppm .pam .exr .nrrd .nhdr .nii .nii.gz .hgt .asc .r16 .r32 .raw";

fn writable(f: Format) -> bool {
    !matches!(f, Format::Dicom | Format::DicomSeries | Format::SliceFolder)
}

/// The same file (device and inode on Unix; the canonical path elsewhere).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
        false
    }
    #[cfg(not(unix))]
    {
        match (a.canonicalize(), b.canonicalize()) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// Split `args` (without the program name) into the command name, the output and the
/// other non-flag arguments (for a command group, its subcommand first).
fn split(args: &[OsString]) -> (Option<String>, Option<PathBuf>, Vec<PathBuf>) {
    let command = args.first().map(|a| a.to_string_lossy().into_owned());
    let mut output = None;
    let mut rest = Vec::new();
    let mut i = 1;
    while i < args.len() {
        let a = &args[i];
        let s = a.to_string_lossy();
        if s == "-o" || s == "--output" {
            output = args.get(i + 1).map(PathBuf::from);
            i += 2;
            continue;
        }
        if let Some(v) = s.strip_prefix("--output=") {
            output = Some(PathBuf::from(v));
        } else if let Some(v) = s.strip_prefix("-o").filter(|_| !s.starts_with("--")) {
            output = Some(PathBuf::from(v.trim_start_matches('=')));
        } else if !s.starts_with('-') || s == "-" {
            rest.push(PathBuf::from(a));
        }
        i += 1;
    }
    (command, output, rest)
}

/// The one format a command writes to `-o -` when `--format` is not given (pictures).
fn std_default(command: &str, subcommand: &str) -> Option<&'static str> {
    match (command, subcommand) {
        ("terrain", "render") | ("mesh", "render") => Some("png"),
        _ => None,
    }
}

/// The value of `--format` in `args`.
fn format_arg(args: &[OsString]) -> Option<String> {
    let mut it = args.iter().map(|a| a.to_string_lossy());
    while let Some(a) = it.next() {
        if a == "--format" {
            return it.next().map(|v| v.into_owned());
        }
        if let Some(v) = a.strip_prefix("--format=") {
            return Some(v.to_string());
        }
    }
    None
}

/// Check `-o -` (standard output) before the command runs: a command whose output
/// format is chosen by the extension needs `--format`, and the format must be one the
/// command writes; a point list is text whatever its extension.
fn check_std(args: &[OsString], command: &str, rest: &[PathBuf]) -> Result<(), Failure> {
    let subcommand = rest
        .first()
        .map(|p| p.to_string_lossy().into_owned())
        .unwrap_or_default();
    let input = match command {
        "denoise" => rest.first().map(PathBuf::as_path),
        _ => None,
    };
    // the commands whose file outputs are not checked by name still need a format here
    let writes = match (command, subcommand.as_str()) {
        ("solid", "polygonize") | ("volume", _) => Writes::Extensions(MESHES),
        ("solid", "voxelize") => Writes::Raster,
        ("solid" | "surface", "render") => Writes::Extensions(&["png"]),
        ("surface", _) => Writes::Extensions(MESHES),
        _ => match expected(command, &subcommand, input) {
            Some(w) => w,
            None => return Ok(()),
        },
    };
    let name = if matches!(command, "mesh" | "curve" | "solid" | "surface" | "volume") {
        format!("{command} {subcommand}")
    } else {
        command.to_string()
    };
    let format = format_arg(args).or_else(|| std_default(command, &subcommand).map(String::from));
    let want = match writes {
        Writes::Extensions(exts) if exts == POINTS => return Ok(()),
        Writes::Extensions([_]) if format.is_none() => return Ok(()),
        Writes::Extensions(exts) => {
            let want: Vec<&str> = exts.to_vec();
            match &format {
                Some(f)
                    if exts.contains(&f.trim_start_matches('.').to_ascii_lowercase().as_str()) =>
                {
                    return Ok(())
                }
                _ => want.join(", "),
            }
        }
        Writes::Raster => {
            let fine = format.as_ref().is_some_and(|f| {
                Format::from_extension(Path::new(&format!("stdout.{}", f.trim_start_matches('.'))))
                    .is_some_and(writable)
            });
            if fine {
                return Ok(());
            }
            RASTER_OUT
                .replace(" .", ", ")
                .trim_start_matches('.')
                .to_string()
        }
    };
    Err(Failure(match format {
        None => format!("standard output: -o - needs --format for {name} ({want})"),
        Some(f) => format!("invalid --format: {f} for {name} (expected {want})"),
    }))
}

/// Check the output of the command line `args` (without the program name).
pub fn check(args: &[OsString]) -> Result<(), Failure> {
    let (command, output, rest) = split(args);
    let Some(out) = output else {
        return Ok(());
    };
    if out.as_os_str() == "-" {
        return check_std(args, command.as_deref().unwrap_or_default(), &rest);
    }
    for input in rest.iter().filter(|p| p.exists()) {
        if out.exists() && same_file(&out, input) {
            return Err(Failure(format!(
                "{}: the output is the input {} (expected a different output file)",
                out.display(),
                input.display()
            )));
        }
    }
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let command = command.unwrap_or_default();
    let subcommand = rest
        .first()
        .map(|p| p.to_string_lossy().into_owned())
        .unwrap_or_default();
    let input = match command.as_str() {
        "denoise" => rest.first().map(PathBuf::as_path),
        _ => None,
    };
    let bad = match expected(&command, &subcommand, input) {
        Some(Writes::Extensions(exts))
            if !exts.iter().any(|e| name.ends_with(&format!(".{e}"))) =>
        {
            let want: Vec<String> = exts.iter().map(|e| format!(".{e}")).collect();
            Some(want.join(" "))
        }
        Some(Writes::Raster) if !Format::from_extension(&out).is_some_and(writable) => {
            Some(format!("one of {RASTER_OUT}"))
        }
        _ => None,
    };
    if let Some(want) = bad {
        return Err(Failure(format!(
            "{}: invalid output extension for {} (expected {want})",
            out.display(),
            if matches!(command.as_str(), "mesh" | "curve") {
                format!("{command} {subcommand}")
            } else {
                command
            },
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn os(v: &[&str]) -> Vec<OsString> {
        v.iter().map(OsString::from).collect()
    }

    #[test]
    fn split_finds_command_output_and_inputs() {
        let (c, o, r) = split(&os(&["encode", "a.png", "-o", "b.mra", "--psnr", "40"]));
        assert_eq!(c.as_deref(), Some("encode"));
        assert_eq!(o, Some(PathBuf::from("b.mra")));
        assert_eq!(r, vec![PathBuf::from("a.png"), PathBuf::from("40")]);
        let (_, o, _) = split(&os(&["decode", "--output=x.png", "a.mra"]));
        assert_eq!(o, Some(PathBuf::from("x.png")));
    }

    #[test]
    fn encode_must_write_mra_and_decode_a_raster() {
        assert!(check(&os(&["encode", "nowhere.png", "-o", "x.png"])).is_err());
        assert!(check(&os(&["encode", "nowhere.png", "-o", "x.MRA"])).is_ok());
        assert!(check(&os(&["decode", "nowhere.mra", "-o", "x.mra"])).is_err());
        assert!(check(&os(&["decode", "nowhere.mra", "-o", "x.jpg"])).is_ok());
        assert!(check(&os(&["decode", "nowhere.mra", "-o", "x.obj"])).is_err());
        assert!(check(&os(&["decode", "nowhere.mra", "-o", "x.nii.gz"])).is_ok());
    }

    #[test]
    fn generate_denoise_mesh_and_curve_outputs_name_what_they_write() {
        assert!(check(&os(&["generate", "zone-plate", "-o", "z.obj"])).is_err());
        assert!(check(&os(&["generate", "zone-plate", "-o", "z.png"])).is_ok());
        assert!(check(&os(&["denoise", "a.csv", "-o", "b.png"])).is_err());
        assert!(check(&os(&["denoise", "a.csv", "-o", "b.csv"])).is_ok());
        assert!(check(&os(&["denoise", "a.png", "-o", "b.csv"])).is_err());
        assert!(check(&os(&["denoise", "a.png", "-o", "b.tif"])).is_ok());
        assert!(check(&os(&["mesh", "smooth", "a.obj", "-o", "b.png"])).is_err());
        assert!(check(&os(&["mesh", "convert", "a.obj", "-o", "b.PLY"])).is_ok());
        assert!(check(&os(&["mesh", "render", "a.obj", "-o", "b.obj"])).is_err());
        assert!(check(&os(&["mesh", "render", "a.obj", "-o", "b.png"])).is_ok());
        assert!(check(&os(&["curve", "plot", "-o", "c.csv"])).is_err());
        assert!(check(&os(&["curve", "plot", "-o", "c.svg"])).is_ok());
        assert!(check(&os(&["curve", "eval", "-o", "c.png"])).is_err());
        assert!(check(&os(&["curve", "eval", "-o", "c.csv"])).is_ok());
        let e = check(&os(&["mesh", "simplify", "a.obj", "-o", "b.stl"])).unwrap_err();
        assert!(
            e.0.contains("mesh simplify") && e.0.contains(".obj .ply .off"),
            "{e}"
        );
    }
}
