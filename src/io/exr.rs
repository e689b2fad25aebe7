//! OpenEXR through the `exr` crate: the first layer, all channels, each channel's
//! stored type (half, float, uint) kept when all channels share it. Channels are
//! ordered R, G, B, A (or Y, A) first, then the rest by name; on output a 1/2/3/4-channel
//! raster gets the names Y / YA / RGB / RGBA.

use std::io::{Seek, Write};
use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, ReadChannels,
    ReadLayers, SmallVec, Vec2, WritableImage,
};

use super::{DataKind, Raster, Samples};
use crate::{Error, Result};

fn exr_error(e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::Io(io)
        }
        exr::error::Error::NotSupported(s) => Error::Unsupported {
            what: "OpenEXR feature",
            value: s.to_string(),
        },
        other => Error::format(format!("invalid OpenEXR: {other}"), "a valid OpenEXR file"),
    }
}

/// Sort key: R G B A / Y A first, others by name.
fn channel_rank(name: &str) -> (usize, String) {
    let r = match name {
        "R" | "Y" => 0,
        "G" => 1,
        "B" => 2,
        "A" => 3,
        _ => 4,
    };
    (r, name.to_string())
}

/// A compressed block inflates at most this many times (ZIP's deflate, the loosest of
/// OpenEXR's codecs, about 1032×): a header declaring more pixel bytes than this
/// multiple of the file's length cannot be real.
const MAX_RATIO: u64 = 1100;

/// Check what the headers of the OpenEXR file at `path` declare before any pixel is
/// allocated: each flat layer's pixel bytes `P = w · h · bytes per pixel` against the
/// file's length (`P ≤ 1100 · len`) and `P + w · h · C · 4` (the crate's channels and
/// the interleaved raster) against the memory budget ([`crate::limits`]).
fn check_declared(path: &Path) -> Result<()> {
    let len = std::fs::metadata(path)?.len();
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(exr_error)?;
    for h in meta.headers.iter().filter(|h| !h.deep) {
        let (w, ht) = (h.layer_size.width() as u64, h.layer_size.height() as u64);
        let area = w.saturating_mul(ht);
        let pixel = area.saturating_mul(h.channels.bytes_per_pixel as u64);
        let most = len.saturating_mul(MAX_RATIO);
        if pixel > most {
            return Err(Error::format(
                format!("OpenEXR header declares {w}x{ht} pixels ({pixel} bytes) but a {len}-byte file holds at most {most}"),
                "a data window the file can hold",
            ));
        }
        let interleaved = area.saturating_mul(h.channels.list.len() as u64 * 4);
        crate::limits::check(
            "decoded image bytes (memory budget MRA_MAX_BYTES)",
            pixel.saturating_add(interleaved),
        )?;
    }
    Ok(())
}

/// Read the first layer of an OpenEXR file as a 2-D raster (its declared size checked
/// first, [`check_declared`]).
pub fn read(path: &Path) -> Result<Raster> {
    check_declared(path)?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(exr_error)?;
    let layer = image.layer_data;
    let (w, h) = (layer.size.x(), layer.size.y());
    let mut chans: Vec<_> = layer.channel_data.list.into_iter().collect();
    chans.sort_by_key(|c| channel_rank(&c.name.to_string()));
    let channels = chans.len();
    let n = w * h;
    let all_f16 = chans
        .iter()
        .all(|c| matches!(c.sample_data, FlatSamples::F16(_)));
    let all_u32 = chans
        .iter()
        .all(|c| matches!(c.sample_data, FlatSamples::U32(_)));
    let samples = if all_f16 {
        let mut out = vec![half::f16::ZERO; n * channels];
        for (ci, c) in chans.iter().enumerate() {
            if let FlatSamples::F16(v) = &c.sample_data {
                for (i, &x) in v.iter().enumerate().take(n) {
                    out[i * channels + ci] = x;
                }
            }
        }
        Samples::F16(out)
    } else if all_u32 {
        let mut out = vec![0u32; n * channels];
        for (ci, c) in chans.iter().enumerate() {
            if let FlatSamples::U32(v) = &c.sample_data {
                for (i, &x) in v.iter().enumerate().take(n) {
                    out[i * channels + ci] = x;
                }
            }
        }
        Samples::U32(out)
    } else {
        let mut out = vec![0f32; n * channels];
        for (ci, c) in chans.iter().enumerate() {
            let vals: Vec<f32> = match &c.sample_data {
                FlatSamples::F16(v) => v.iter().map(|x| x.to_f32()).collect(),
                FlatSamples::F32(v) => v.clone(),
                FlatSamples::U32(v) => v.iter().map(|&x| x as f32).collect(),
            };
            for (i, &x) in vals.iter().enumerate().take(n) {
                out[i * channels + ci] = x;
            }
        }
        Samples::F32(out)
    };
    Raster::new(vec![h, w], channels, samples, DataKind::Image)
}

/// Write a 2-D f16 / f32 / u32 raster (1–4 channels, or more named C0, C1, …) as
/// OpenEXR with lossless ZIP compression.
pub fn write<W: Write + Seek>(w: &mut W, r: &Raster) -> Result<()> {
    if r.dims.len() != 2 {
        return Err(Error::Unsupported {
            what: "OpenEXR output",
            value: format!("{}-D data (expected 2-D)", r.dims.len()),
        });
    }
    let names: Vec<String> = match r.channels {
        1 => vec!["Y".into()],
        2 => vec!["Y".into(), "A".into()],
        3 => vec!["R".into(), "G".into(), "B".into()],
        4 => vec!["R".into(), "G".into(), "B".into(), "A".into()],
        c => (0..c).map(|i| format!("C{i}")).collect(),
    };
    let c = r.channels;
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (ci, name) in names.iter().enumerate() {
        let data = match &r.samples {
            Samples::F16(v) => FlatSamples::F16(v.iter().skip(ci).step_by(c).copied().collect()),
            Samples::F32(v) => FlatSamples::F32(v.iter().skip(ci).step_by(c).copied().collect()),
            Samples::U32(v) => FlatSamples::U32(v.iter().skip(ci).step_by(c).copied().collect()),
            other => {
                return Err(Error::Unsupported {
                    what: "OpenEXR output",
                    value: format!("{} samples (expected f16, f32 or u32)", other.sample_type()),
                })
            }
        };
        list.push(AnyChannel::new(name.as_str(), data));
    }
    let layer = Layer::new(
        Vec2(r.width(), r.height()),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer)
        .write()
        .to_buffered(w)
        .map_err(exr_error)
}
