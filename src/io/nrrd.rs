//! NRRD (Teem's "nearly raw raster data"): a text header, a blank line, then the data —
//! or a detached header (`.nhdr`) whose `data file:` names the data. Encodings raw,
//! gzip and ascii; both byte orders; the first axis becomes the channel axis when its
//! `kinds` entry is a colour / vector kind. Axes are stored fastest first (`sizes: nx ny
//! nz`), so `dims` is `sizes` reversed.
//!
//! Kept: `space`, `space directions` (spacing = length of each direction), `space origin`,
//! `spacings`, `space units`, `content`, and every `key:=value` pair (into
//! [`Metadata::extra`](super::Metadata)). Written: NRRD0005 with the same fields.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use flate2::read::MultiGzDecoder;

use super::bytes::{self, checked_bytes, sample_count};
use super::slab::{FileSlabs, Shape};
use super::{DataKind, Metadata, Raster, SampleType, Samples};
use crate::{Error, Result};

/// The parsed header, before reading data.
#[derive(Debug, Default)]
struct Header {
    sample_type: Option<SampleType>,
    sizes: Vec<usize>,
    kinds: Vec<String>,
    big_endian: bool,
    encoding: String,
    data_file: Option<String>,
    byte_skip: i64,
    line_skip: usize,
    meta: Metadata,
}

fn nrrd_type(s: &str) -> Result<SampleType> {
    Ok(match s.trim() {
        "signed char" | "int8" | "int8_t" => SampleType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => SampleType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            SampleType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
            SampleType::U16
        }
        "int" | "signed int" | "int32" | "int32_t" => SampleType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => SampleType::U32,
        "float" => SampleType::F32,
        "double" => SampleType::F64,
        other => {
            return Err(Error::Unsupported {
                what: "NRRD type",
                value: other.to_string(),
            })
        }
    })
}

fn type_name(t: SampleType) -> Result<&'static str> {
    Ok(match t {
        SampleType::I8 => "int8",
        SampleType::U8 => "uint8",
        SampleType::I16 => "int16",
        SampleType::U16 => "uint16",
        SampleType::I32 => "int32",
        SampleType::U32 => "uint32",
        SampleType::F32 => "float",
        SampleType::F64 => "double",
        SampleType::F16 => {
            return Err(Error::Unsupported {
                what: "NRRD output",
                value: "f16 samples (NRRD has no half type; use .exr or convert to f32)".into(),
            })
        }
    })
}

/// Kinds that make the first axis a channel axis.
fn is_channel_kind(k: &str) -> bool {
    let k = k.to_ascii_lowercase();
    matches!(
        k.as_str(),
        "rgb-color"
            | "rgba-color"
            | "hsv-color"
            | "xyz-color"
            | "2-vector"
            | "3-vector"
            | "4-vector"
            | "3-color"
            | "4-color"
            | "vector"
            | "covariant-vector"
            | "normal"
            | "list"
            | "point"
            | "complex"
            | "3-gradient"
            | "3-normal"
    )
}

/// Parse a vector like `(1.5,0,0)`; `none` gives `None`.
fn parse_vector(s: &str) -> Option<Vec<f64>> {
    let s = s.trim();
    let inner = s.strip_prefix('(')?.strip_suffix(')')?;
    inner.split(',').map(|t| t.trim().parse().ok()).collect()
}

/// Split `(a,b,c) none (d,e,f)` into items.
fn split_vectors(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut depth = 0;
    for ch in s.chars() {
        match ch {
            '(' => {
                depth += 1;
                cur.push(ch);
            }
            ')' => {
                depth -= 1;
                cur.push(ch);
            }
            c if c.is_whitespace() && depth == 0 => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
            }
            c => cur.push(c),
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

fn bad(what: impl std::fmt::Display) -> Error {
    Error::format(what, "a valid NRRD header")
}

/// Parse the header text (without the magic line's trailing data).
fn parse_header(text: &str) -> Result<Header> {
    let mut lines = text.lines();
    let magic = lines.next().unwrap_or("");
    if !magic.starts_with("NRRD000") {
        return Err(bad("missing NRRD000x magic line"));
    }
    let mut h = Header {
        encoding: "raw".into(),
        ..Default::default()
    };
    let mut dimension = None;
    let mut directions: Option<Vec<String>> = None;
    let mut spacings: Option<Vec<String>> = None;
    for line in lines {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        if let Some((k, v)) = line.split_once(":=") {
            h.meta.extra.insert(k.to_string(), v.to_string());
            continue;
        }
        let Some((field, value)) = line.split_once(": ") else {
            return Err(bad(format!("header line without 'field: value': {line:?}")));
        };
        let value = value.trim();
        match field.trim().to_ascii_lowercase().as_str() {
            "type" => h.sample_type = Some(nrrd_type(value)?),
            "dimension" => {
                dimension = Some(
                    value
                        .parse::<usize>()
                        .map_err(|_| bad(format!("dimension {value:?}")))?,
                )
            }
            "sizes" => {
                h.sizes = value
                    .split_whitespace()
                    .map(|t| t.parse::<usize>().map_err(|_| bad(format!("size {t:?}"))))
                    .collect::<Result<_>>()?
            }
            "endian" => h.big_endian = value == "big",
            "encoding" => h.encoding = value.to_ascii_lowercase(),
            "data file" | "datafile" => h.data_file = Some(value.to_string()),
            "byte skip" | "byteskip" => {
                h.byte_skip = value
                    .parse()
                    .map_err(|_| bad(format!("byte skip {value:?}")))?
            }
            "line skip" | "lineskip" => {
                h.line_skip = value
                    .parse()
                    .map_err(|_| bad(format!("line skip {value:?}")))?
            }
            "kinds" => h.kinds = value.split_whitespace().map(String::from).collect(),
            "space" => h.meta.space = Some(value.to_string()),
            "space dimension" => {}
            "space directions" => directions = Some(split_vectors(value)),
            "space origin" => h.meta.origin = parse_vector(value),
            "spacings" => spacings = Some(value.split_whitespace().map(String::from).collect()),
            "space units" => {
                h.meta.units = value
                    .split('"')
                    .map(str::trim)
                    .find(|s| !s.is_empty())
                    .map(String::from)
            }
            "content" => h.meta.description = Some(value.to_string()),
            _ => {
                h.meta
                    .extra
                    .insert(format!("nrrd.{field}"), value.to_string());
            }
        }
    }
    if let Some(nd) = h.meta.extra.remove("mra.nodata") {
        h.meta.nodata = nd.trim().parse().ok();
    }
    if h.sample_type.is_none() {
        return Err(bad("no 'type' field"));
    }
    let dim = dimension.ok_or_else(|| bad("no 'dimension' field"))?;
    if h.sizes.len() != dim || dim == 0 {
        return Err(bad(format!("dimension {dim} but {} sizes", h.sizes.len())));
    }
    if !h.kinds.is_empty() && h.kinds.len() != dim {
        return Err(bad(format!("dimension {dim} but {} kinds", h.kinds.len())));
    }
    set_spacing(&mut h, dim, directions, spacings);
    Ok(h)
}

impl Header {
    /// Channels and spatial dims (slowest first): a channel axis is a first axis of a
    /// channel kind (in a header of two or more dimensions).
    fn layout(&self) -> (usize, Vec<usize>) {
        let h = self;
        let dim = h.sizes.len();
        let chan_axis = dim >= 2 && h.kinds.first().is_some_and(|k| is_channel_kind(k));
        let (channels, spatial) = if chan_axis {
            (h.sizes[0], &h.sizes[1..])
        } else {
            (1, &h.sizes[..])
        };
        (channels, spatial.iter().rev().copied().collect())
    }
}

/// Spacing (slowest axis first) and directions from `space directions` (spacing = each
/// vector's length) or else `spacings`, over the spatial axes (all but a channel axis in
/// first position); left unset when they do not match the dimension.
fn set_spacing(
    h: &mut Header,
    dim: usize,
    directions: Option<Vec<String>>,
    spacings: Option<Vec<String>>,
) {
    let chan_axis = dim >= 2 && h.kinds.first().is_some_and(|k| is_channel_kind(k));
    let first = usize::from(chan_axis);
    if let Some(dirs) = directions {
        if dirs.len() == dim {
            let vecs: Vec<Vec<f64>> = dirs[first..]
                .iter()
                .filter_map(|d| parse_vector(d))
                .collect();
            if vecs.len() == dim - first {
                let mut sp: Vec<f64> = vecs
                    .iter()
                    .map(|v| v.iter().map(|x| x * x).sum::<f64>().sqrt())
                    .collect();
                sp.reverse();
                h.meta.spacing = Some(sp);
                h.meta.directions = Some(vecs);
            }
        }
    } else if let Some(sps) = spacings {
        if sps.len() == dim {
            let sp: Option<Vec<f64>> = sps[first..].iter().map(|s| s.parse().ok()).collect();
            if let Some(mut sp) = sp {
                sp.reverse();
                h.meta.spacing = Some(sp);
            }
        }
    }
}

/// The samples of `payload` (after line skips) by the header's encoding and byte skip.
fn decode_payload(
    h: &Header,
    mut payload: &[u8],
    dims: &[usize],
    channels: usize,
) -> Result<Samples> {
    let n = sample_count(dims, channels)?;
    let ty = h.sample_type.expect("checked");
    Ok(match h.encoding.as_str() {
        "raw" => {
            let need = if h.byte_skip == -1 {
                let need = checked_bytes(dims, channels, ty, payload.len() as u64)?;
                payload = &payload[payload.len() - need..];
                need
            } else {
                let skip = h.byte_skip.max(0) as usize;
                payload = payload.get(skip..).unwrap_or(&[]);
                checked_bytes(dims, channels, ty, payload.len() as u64)?
            };
            bytes::decode(&payload[..need], ty, h.big_endian)
        }
        "gzip" | "gz" => {
            let need = checked_bytes(dims, channels, ty, u64::MAX)?;
            let skip = h.byte_skip.max(0) as usize;
            if skip > 0 {
                return Err(Error::Unsupported {
                    what: "NRRD byte skip",
                    value: "with gzip encoding".into(),
                });
            }
            // deflate expands one byte to at most 1032 (258-byte matches in 2 bits): a
            // declared size the stream cannot hold is refused before the buffer is made
            let most = (payload.len() as u64).saturating_mul(1032).max(1 << 16);
            if need as u64 > most {
                return Err(Error::format(
                    format!(
                        "header declares {need} bytes of data but a {}-byte gzip stream inflates to at most {most}",
                        payload.len()
                    ),
                    "a data size that fits the file",
                ));
            }
            // inflated straight into the samples' buffer (the size checked above)
            bytes::read_samples(MultiGzDecoder::new(payload), n, ty, h.big_endian).map_err(|e| {
                match e.kind() {
                    std::io::ErrorKind::UnexpectedEof => Error::format(
                        format!(
                            "header declares {need} bytes of data but the gzip stream ends before"
                        ),
                        "a data size that fits the file",
                    ),
                    _ => Error::format(format!("gzip data: {e}"), "valid gzip-encoded NRRD data"),
                }
            })?
        }
        "ascii" | "text" | "txt" => {
            let text = std::str::from_utf8(payload).map_err(|_| bad("ascii data is not text"))?;
            let vals: Vec<f64> = text
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|t| !t.is_empty())
                .take(n)
                .map(|t| {
                    t.parse::<f64>()
                        .map_err(|_| bad(format!("ascii value {t:?}")))
                })
                .collect::<Result<_>>()?;
            if vals.len() < n {
                return Err(bad(format!("{} ascii values for {n} samples", vals.len())));
            }
            Samples::from_f64(&vals, ty)
        }
        other => {
            return Err(Error::Unsupported {
                what: "NRRD encoding",
                value: other.to_string(),
            })
        }
    })
}

/// Read an attached (`.nrrd`) or detached (`.nhdr`) NRRD file.
pub fn read(path: &Path) -> Result<Raster> {
    let file = bytes::read_all(path)?;
    // header ends at the first empty line (attached) or at the end of the file (detached)
    let (head_end, data_start) = match find_blank_line(&file) {
        Some((a, b)) => (a, b),
        None => (file.len(), file.len()),
    };
    let text = std::str::from_utf8(&file[..head_end]).map_err(|_| bad("header is not text"))?;
    let h = parse_header(text)?;
    let ty = h.sample_type.expect("checked");
    let (channels, dims) = h.layout();

    // the decoded size, checked against the memory budget before any data is read
    let budget = crate::limits::Limits::from_env()?;
    let need_bytes = (sample_count(&dims, channels)? as u64).saturating_mul(ty.size() as u64);
    budget.check("NRRD data bytes (memory budget MRA_MAX_BYTES)", need_bytes)?;

    // the bytes holding the (possibly encoded) data
    let detached;
    let payload: &[u8] = match &h.data_file {
        Some(name) if name != "LIST" && !name.contains('%') => {
            let p: PathBuf = path.parent().unwrap_or(Path::new(".")).join(name);
            // raw data at a known offset: exactly the bytes the header needs
            let exact = (h.encoding == "raw" && h.byte_skip >= 0 && h.line_skip == 0)
                .then(|| need_bytes.saturating_add(h.byte_skip as u64));
            detached = read_data_file(&p, exact, budget.max_bytes)?;
            &detached
        }
        Some(other) => {
            return Err(Error::Unsupported {
                what: "NRRD data file",
                value: other.clone(),
            })
        }
        None => {
            if data_start >= file.len() && head_end == file.len() {
                return Err(bad("no blank line after the header and no 'data file'"));
            }
            &file[data_start..]
        }
    };
    let mut payload = payload;
    for _ in 0..h.line_skip {
        match payload.iter().position(|&b| b == b'\n') {
            Some(i) => payload = &payload[i + 1..],
            None => return Err(bad("line skip beyond the end of the data")),
        }
    }

    let samples = decode_payload(&h, payload, &dims, channels)?;
    let kind = match dims.len() {
        1 => DataKind::Sequence,
        2 => DataKind::Image,
        _ => DataKind::Volume,
    };
    let mut r = Raster::new(dims, channels, samples, kind)?;
    r.meta = h.meta;
    Ok(r)
}

/// A NRRD of raw encoding (attached, or detached with a plain data file name) as a
/// source of slabs, its samples read by seeking; `None` for any other encoding or
/// layout (line skips, data file lists), which [`read`] reads whole.
pub fn open_slabs(path: &Path) -> Result<Option<FileSlabs>> {
    // the header: up to its blank line, or the whole of a detached header
    const MOST: u64 = 1 << 20;
    let mut head = Vec::new();
    std::fs::File::open(path)?
        .take(MOST)
        .read_to_end(&mut head)?;
    let len = std::fs::metadata(path)?.len();
    let (head_end, data_start) = match find_blank_line(&head) {
        Some(p) => p,
        None if (head.len() as u64) == len => (head.len(), head.len()),
        None => return Ok(None),
    };
    let text = std::str::from_utf8(&head[..head_end]).map_err(|_| bad("header is not text"))?;
    let h = parse_header(text)?;
    if h.encoding != "raw" || h.line_skip != 0 || h.byte_skip < -1 {
        return Ok(None);
    }
    let ty = h.sample_type.expect("checked");
    let (channels, dims) = h.layout();
    let (data, start) = match &h.data_file {
        None if data_start == head_end && head_end as u64 == len => {
            return Err(bad("no blank line after the header and no 'data file'"))
        }
        None => (path.to_path_buf(), data_start as u64),
        Some(name) if name != "LIST" && !name.contains('%') => {
            let p = path.parent().unwrap_or(Path::new(".")).join(name);
            if !std::fs::metadata(&p)?.is_file() {
                return Ok(None);
            }
            (p, 0)
        }
        Some(_) => return Ok(None),
    };
    let data_len = std::fs::metadata(&data)?.len();
    let need = checked_bytes(&dims, channels, ty, data_len.saturating_sub(start))? as u64;
    let offset = if h.byte_skip == -1 {
        data_len - need
    } else {
        let o = start + h.byte_skip as u64;
        checked_bytes(&dims, channels, ty, data_len.saturating_sub(o))?;
        o
    };
    let kind = match dims.len() {
        1 => DataKind::Sequence,
        2 => DataKind::Image,
        _ => DataKind::Volume,
    };
    let shape = Shape {
        dims,
        channels,
        sample_type: ty,
        kind,
        meta: h.meta,
    };
    FileSlabs::new(shape, &data, offset, h.big_endian).map(Some)
}

/// Read a detached data file: at most `exact` bytes when the header fixes how many it
/// needs (a regular file or a character device such as `/dev/zero`), else the whole of a
/// regular file of at most `max` bytes. A FIFO, socket or folder is refused before it is
/// opened (opening a FIFO blocks until a writer appears, and its data may never end).
fn read_data_file(p: &Path, exact: Option<u64>, max: u64) -> Result<Vec<u8>> {
    let md = std::fs::metadata(p)?;
    let ft = md.file_type();
    #[cfg(unix)]
    let device = {
        use std::os::unix::fs::FileTypeExt;
        ft.is_char_device() || ft.is_block_device()
    };
    #[cfg(not(unix))]
    let device = false;
    let limit = match exact {
        Some(n) if ft.is_file() || device => n,
        None if ft.is_file() => {
            if md.len() > max {
                return Err(Error::LimitsExceeded {
                    what: "NRRD data file bytes (memory budget MRA_MAX_BYTES)",
                    requested: md.len(),
                    limit: max,
                });
            }
            md.len()
        }
        _ => {
            return Err(Error::Unsupported {
                what: "NRRD data file",
                value: format!(
                    "{} is not a regular file (expected a regular file, or a device for raw data at a fixed offset)",
                    p.display()
                ),
            })
        }
    };
    let f = std::fs::File::open(p)?;
    let cap = if ft.is_file() {
        limit.min(md.len())
    } else {
        limit
    };
    let mut v = Vec::with_capacity(cap as usize);
    f.take(limit).read_to_end(&mut v)?;
    Ok(v)
}

/// Index of the end of the header and the start of the data (after `\n\n` or `\r\n\r\n`).
fn find_blank_line(b: &[u8]) -> Option<(usize, usize)> {
    let mut i = 0;
    while i + 1 < b.len() {
        if b[i] == b'\n' {
            if b[i + 1] == b'\n' {
                return Some((i + 1, i + 2));
            }
            if b[i + 1] == b'\r' && b.get(i + 2) == Some(&b'\n') {
                return Some((i + 1, i + 3));
            }
        }
        i += 1;
    }
    None
}

/// The header text for `r` (ending with a newline, without the blank separator line).
pub(super) fn header_text(r: &Shape, encoding: &str, data_file: Option<&str>) -> Result<String> {
    let ty = type_name(r.sample_type)?;
    let mut sizes: Vec<usize> = r.dims.iter().rev().copied().collect();
    let mut kinds: Vec<&str> = vec!["domain"; sizes.len()];
    let chan = r.channels > 1;
    if chan {
        sizes.insert(0, r.channels);
        kinds.insert(
            0,
            match r.channels {
                3 => "RGB-color",
                4 => "RGBA-color",
                _ => "vector",
            },
        );
    }
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let mut s = String::from("NRRD0005\n# written by mra\n");
    s += &format!("type: {ty}\ndimension: {}\n", sizes.len());
    if let Some(space) = &r.meta.space {
        s += &format!("space: {space}\n");
    }
    s += &format!(
        "sizes: {}\n",
        sizes
            .iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    let ndirs = r.dims.len();
    let dirs: Option<Vec<Vec<f64>>> = match (&r.meta.directions, &r.meta.spacing) {
        (Some(d), _) if d.len() == ndirs => Some(d.clone()),
        (_, Some(sp)) if sp.len() == ndirs && r.meta.space.is_some() => Some(
            (0..ndirs)
                .map(|i| {
                    let mut v = vec![0.0; ndirs];
                    v[i] = sp[ndirs - 1 - i];
                    v
                })
                .collect(),
        ),
        _ => None,
    };
    if let (Some(d), true) = (&dirs, r.meta.space.is_some()) {
        let mut items: Vec<String> = d.iter().map(|v| format!("({})", join(v))).collect();
        if chan {
            items.insert(0, "none".into());
        }
        s += &format!("space directions: {}\n", items.join(" "));
    } else if let Some(sp) = &r.meta.spacing {
        if sp.len() == ndirs {
            let mut items: Vec<String> = sp.iter().rev().map(|x| format!("{x}")).collect();
            if chan {
                items.insert(0, "nan".into());
            }
            s += &format!("spacings: {}\n", items.join(" "));
        }
    }
    s += &format!("kinds: {}\n", kinds.join(" "));
    if r.sample_type.size() > 1 {
        s += "endian: little\n";
    }
    s += &format!("encoding: {encoding}\n");
    if let (Some(o), true) = (&r.meta.origin, r.meta.space.is_some()) {
        s += &format!("space origin: ({})\n", join(o));
    }
    if let Some(u) = &r.meta.units {
        if r.meta.space.is_some() {
            let us: Vec<String> = (0..ndirs).map(|_| format!("\"{u}\"")).collect();
            s += &format!("space units: {}\n", us.join(" "));
        }
    }
    if let Some(c) = &r.meta.description {
        s += &format!("content: {}\n", c.replace('\n', " "));
    }
    if let Some(df) = data_file {
        s += &format!("data file: {df}\n");
    }
    for (k, v) in &r.meta.extra {
        if k.starts_with("nrrd.") || k == "mra.nodata" || k.contains(":=") || k.contains('\n') {
            continue;
        }
        s += &format!("{k}:={}\n", v.replace('\n', "\\n"));
    }
    if let Some(nd) = r.meta.nodata {
        s += &format!("mra.nodata:={nd}\n");
    }
    Ok(s)
}

fn payload(r: &Raster, gzip: bool) -> Result<Vec<u8>> {
    let raw = bytes::encode(&r.samples, false);
    if !gzip {
        return Ok(raw);
    }
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(&raw)?;
    Ok(enc.finish()?)
}

/// Write an attached NRRD (header, blank line, data) into `w`.
pub fn write<W: Write>(w: &mut W, r: &Raster, gzip: bool) -> Result<()> {
    let head = header_text(&Shape::of(r), if gzip { "gzip" } else { "raw" }, None)?;
    w.write_all(head.as_bytes())?;
    w.write_all(b"\n")?;
    w.write_all(&payload(r, gzip)?)?;
    Ok(())
}

/// Write `path`: `.nrrd` attached; `.nhdr` detached with the data beside it in
/// `NAME.raw` (or `NAME.raw.gz` when compressed). Both files appear only when complete.
pub fn write_path(path: &Path, r: &Raster, gzip: bool) -> Result<()> {
    let detached = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("nhdr"));
    if !detached {
        return bytes::atomic_write(path, |w| write(w, r, gzip));
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "data".into());
    let data_name = format!("{stem}.raw{}", if gzip { ".gz" } else { "" });
    let data_path = path.with_file_name(&data_name);
    let head = header_text(
        &Shape::of(r),
        if gzip { "gzip" } else { "raw" },
        Some(&data_name),
    )?;
    let data = payload(r, gzip)?;
    bytes::atomic_write(&data_path, |w| Ok(w.write_all(&data)?))?;
    let res = bytes::atomic_write(path, |w| Ok(w.write_all(head.as_bytes())?));
    if res.is_err() {
        let _ = std::fs::remove_file(&data_path);
    }
    res
}
