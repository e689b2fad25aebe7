//! Byte-level helpers shared by the readers and writers: sizes checked before any
//! allocation, endian decoding and encoding of sample arrays, and atomic writes
//! (temporary file in the same folder, renamed when complete).

use std::fs::File;
use std::io::{BufWriter, Read};
use std::path::Path;

use byteorder::{BigEndian, ByteOrder, LittleEndian};

use super::{SampleType, Samples, MAX_SAMPLES};
use crate::{Error, Result};

/// Read up to `buf.len()` bytes from the start of `path`; returns how many were read.
pub fn read_head(path: &Path, buf: &mut [u8]) -> Result<usize> {
    let mut f = File::open(path)?;
    let mut n = 0;
    while n < buf.len() {
        let k = f.read(&mut buf[n..])?;
        if k == 0 {
            break;
        }
        n += k;
    }
    Ok(n)
}

/// `dims[0] × dims[1] × … × channels`, or [`Error::LimitsExceeded`] when it overflows or
/// exceeds [`MAX_SAMPLES`].
pub fn sample_count(dims: &[usize], channels: usize) -> Result<usize> {
    let mut n: u64 = channels as u64;
    for &d in dims {
        n = n.checked_mul(d as u64).ok_or(Error::LimitsExceeded {
            what: "sample count",
            requested: u64::MAX,
            limit: MAX_SAMPLES,
        })?;
    }
    if n > MAX_SAMPLES {
        return Err(Error::LimitsExceeded {
            what: "sample count",
            requested: n,
            limit: MAX_SAMPLES,
        });
    }
    Ok(n as usize)
}

/// Bytes needed for `dims × channels` samples of `ty`, checked against `available`
/// (what the file holds) before anything is allocated.
pub fn checked_bytes(
    dims: &[usize],
    channels: usize,
    ty: SampleType,
    available: u64,
) -> Result<usize> {
    let n = sample_count(dims, channels)?;
    let need = (n as u64)
        .checked_mul(ty.size() as u64)
        .ok_or(Error::LimitsExceeded {
            what: "data size",
            requested: u64::MAX,
            limit: MAX_SAMPLES,
        })?;
    if need > available {
        return Err(Error::format(
            format!(
                "header declares {need} bytes of data ({} × {} channels × {} bytes) but the file holds {available}",
                dims.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("×"),
                channels,
                ty.size()
            ),
            "a data size that fits the file",
        ));
    }
    Ok(need as usize)
}

/// Decode `bytes` (exactly `n × ty.size()` long) as samples of `ty`.
pub fn decode(bytes: &[u8], ty: SampleType, big_endian: bool) -> Samples {
    fn conv<T, F: Fn(&[u8]) -> T>(b: &[u8], size: usize, f: F) -> Vec<T> {
        b.chunks_exact(size).map(f).collect()
    }
    macro_rules! endian {
        ($read:ident) => {
            if big_endian {
                |c: &[u8]| BigEndian::$read(c)
            } else {
                |c: &[u8]| LittleEndian::$read(c)
            }
        };
    }
    match ty {
        SampleType::U8 => Samples::U8(bytes.to_vec()),
        SampleType::I8 => Samples::I8(bytes.iter().map(|&b| b as i8).collect()),
        SampleType::U16 => Samples::U16(conv(bytes, 2, endian!(read_u16))),
        SampleType::I16 => Samples::I16(conv(bytes, 2, endian!(read_i16))),
        SampleType::U32 => Samples::U32(conv(bytes, 4, endian!(read_u32))),
        SampleType::I32 => Samples::I32(conv(bytes, 4, endian!(read_i32))),
        SampleType::F16 => {
            let bits: Vec<u16> = conv(bytes, 2, endian!(read_u16));
            Samples::F16(bits.into_iter().map(half::f16::from_bits).collect())
        }
        SampleType::F32 => Samples::F32(conv(bytes, 4, endian!(read_f32))),
        SampleType::F64 => Samples::F64(conv(bytes, 8, endian!(read_f64))),
    }
}

/// `n` samples of type `ty` read from `r` straight into their typed buffer (no byte
/// buffer in between: a decoded volume costs one array, not two). A stream ending
/// before `n` samples is `UnexpectedEof`. The caller checks `n` against the budget.
pub fn read_samples<R: std::io::Read>(
    r: R,
    n: usize,
    ty: SampleType,
    big_endian: bool,
) -> std::io::Result<Samples> {
    struct Stream<R>(R, bool);
    impl<R: Read> FillSamples for Stream<R> {
        type Error = std::io::Error;
        fn fill<T: ReadInto>(&mut self, v: &mut [T]) -> std::io::Result<()> {
            T::read_into(&mut self.0, self.1, v)
        }
    }
    typed_samples(ty, n, &mut Stream(r, big_endian))
}

/// A sample element read from a byte stream in either byte order.
pub(crate) trait ReadInto: Copy + Default + Send + Sync + 'static {
    fn read_into<R: Read>(r: &mut R, big_endian: bool, v: &mut [Self]) -> std::io::Result<()>;
}

impl ReadInto for u8 {
    fn read_into<R: Read>(r: &mut R, _: bool, v: &mut [u8]) -> std::io::Result<()> {
        r.read_exact(v)
    }
}

impl ReadInto for i8 {
    fn read_into<R: Read>(r: &mut R, _: bool, v: &mut [i8]) -> std::io::Result<()> {
        byteorder::ReadBytesExt::read_i8_into(r, v)
    }
}

macro_rules! read_into {
    ($($t:ty: $read:ident),*) => {$(
        impl ReadInto for $t {
            fn read_into<R: Read>(r: &mut R, big_endian: bool, v: &mut [$t]) -> std::io::Result<()> {
                use byteorder::ReadBytesExt;
                if big_endian {
                    r.$read::<BigEndian>(v)
                } else {
                    r.$read::<LittleEndian>(v)
                }
            }
        }
    )*};
}
read_into!(u16: read_u16_into, i16: read_i16_into, u32: read_u32_into, i32: read_i32_into,
    f32: read_f32_into, f64: read_f64_into);

/// How a reader fills a typed sample buffer (one stream, or pieces read in parallel).
pub(crate) trait FillSamples {
    type Error;
    fn fill<T: ReadInto>(&mut self, v: &mut [T]) -> std::result::Result<(), Self::Error>;
}

/// `n` samples of type `ty`, their buffer (zeroed, on huge pages where allowed) filled by `f`;
/// `f16` is read as its bits.
pub(crate) fn typed_samples<F: FillSamples>(
    ty: SampleType,
    n: usize,
    f: &mut F,
) -> std::result::Result<Samples, F::Error> {
    fn buf<T: ReadInto, F: FillSamples>(
        n: usize,
        f: &mut F,
    ) -> std::result::Result<Vec<T>, F::Error> {
        let mut v: Vec<T> = crate::tensor::zeroed_vec(n);
        f.fill(&mut v)?;
        Ok(v)
    }
    Ok(match ty {
        SampleType::U8 => Samples::U8(buf(n, f)?),
        SampleType::I8 => Samples::I8(buf(n, f)?),
        SampleType::U16 => Samples::U16(buf(n, f)?),
        SampleType::I16 => Samples::I16(buf(n, f)?),
        SampleType::U32 => Samples::U32(buf(n, f)?),
        SampleType::I32 => Samples::I32(buf(n, f)?),
        SampleType::F16 => {
            let bits: Vec<u16> = buf(n, f)?;
            Samples::F16(bits.into_iter().map(half::f16::from_bits).collect())
        }
        SampleType::F32 => Samples::F32(buf(n, f)?),
        SampleType::F64 => Samples::F64(buf(n, f)?),
    })
}

/// Encode samples as bytes in the given byte order.
pub fn encode(s: &Samples, big_endian: bool) -> Vec<u8> {
    macro_rules! enc {
        ($v:expr, $size:expr, $write:ident) => {{
            let mut out = vec![0u8; $v.len() * $size];
            for (c, &x) in out.chunks_exact_mut($size).zip($v.iter()) {
                if big_endian {
                    BigEndian::$write(c, x);
                } else {
                    LittleEndian::$write(c, x);
                }
            }
            out
        }};
    }
    match s {
        Samples::U8(v) => v.clone(),
        Samples::I8(v) => v.iter().map(|&x| x as u8).collect(),
        Samples::U16(v) => enc!(v, 2, write_u16),
        Samples::I16(v) => enc!(v, 2, write_i16),
        Samples::U32(v) => enc!(v, 4, write_u32),
        Samples::I32(v) => enc!(v, 4, write_i32),
        Samples::F16(v) => {
            let bits: Vec<u16> = v.iter().map(|x| x.to_bits()).collect();
            enc!(bits, 2, write_u16)
        }
        Samples::F32(v) => enc!(v, 4, write_f32),
        Samples::F64(v) => enc!(v, 8, write_f64),
    }
}

/// The bytes of samples `r` of `s` (as [`encode`] gives them) into `out`, replacing its
/// contents: a reused buffer instead of a copy of the samples and a fresh vector.
pub fn encode_into(s: &Samples, r: std::ops::Range<usize>, big_endian: bool, out: &mut Vec<u8>) {
    macro_rules! enc {
        ($v:expr, $size:expr, $write:ident) => {{
            let v = &$v[r];
            out.clear();
            out.resize(v.len() * $size, 0);
            for (c, &x) in out.chunks_exact_mut($size).zip(v.iter()) {
                if big_endian {
                    BigEndian::$write(c, x);
                } else {
                    LittleEndian::$write(c, x);
                }
            }
        }};
    }
    match s {
        Samples::U8(v) => {
            out.clear();
            out.extend_from_slice(&v[r]);
        }
        Samples::I8(v) => {
            out.clear();
            out.extend(v[r].iter().map(|&x| x as u8));
        }
        Samples::U16(v) => enc!(v, 2, write_u16),
        Samples::I16(v) => enc!(v, 2, write_i16),
        Samples::U32(v) => enc!(v, 4, write_u32),
        Samples::I32(v) => enc!(v, 4, write_i32),
        Samples::F16(v) => {
            out.clear();
            out.resize(v[r.clone()].len() * 2, 0);
            for (c, x) in out.chunks_exact_mut(2).zip(&v[r]) {
                if big_endian {
                    BigEndian::write_u16(c, x.to_bits());
                } else {
                    LittleEndian::write_u16(c, x.to_bits());
                }
            }
        }
        Samples::F32(v) => enc!(v, 4, write_f32),
        Samples::F64(v) => enc!(v, 8, write_f64),
    }
}

/// Write through `body` into a temporary file beside `path`, then rename it onto
/// `path` ([`crate::fsutil::write_atomic`]).
pub fn atomic_write<F>(path: &Path, body: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<()>,
{
    crate::fsutil::write_atomic(path, body)
}

/// Read a whole file, refusing files larger than `limit` bytes.
pub fn read_all(path: &Path) -> Result<Vec<u8>> {
    Ok(std::fs::read(path)?)
}
