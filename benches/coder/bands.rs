//! The quantized bands of a `.mra` file as today's encoder wrote them, for measuring
//! coefficient coders on real data: the `HEAD` and `LEVL` chunks of a one-piece format 2
//! file read, the bands planned as the codec plans them (non-standard pyramid, or the
//! integer one of a lossless file; a band's parent is the band one level coarser with
//! the same orientation), and every band's stream decoded by `entropy::band`.

#![allow(dead_code)]

use mra::codec::lossless;
use mra::entropy::band::{self, Classes, Coding};
use mra::entropy::range::{Decoder, Encoder};
use mra::entropy::{BandKind, Parent};
use mra::format::{ChunkReader, Cursor, Header, Mode};
use mra::tensor::{Order, Pyramid, PyramidSpec};
use mra::{Error, Result};

/// One band of one channel.
pub struct Band {
    pub level: usize,
    pub channel: usize,
    pub kind: BandKind,
    pub dims: Vec<usize>,
    /// the index (in [`Bands::bands`]) of its parent band
    pub parent: Option<usize>,
    /// the indices, as decoded
    pub q: Vec<i64>,
    /// the same indices as `i32`
    pub q32: Vec<i32>,
    /// today's stream of the band, as in the file
    pub stream: Vec<u8>,
}

/// The bands of a file and what they came from.
pub struct Bands {
    pub header: Header,
    pub coding: Coding,
    pub bands: Vec<Band>,
    /// bytes of the raw samples (positions × channels × sample size)
    pub raw_bytes: usize,
}

impl Bands {
    /// The bands of a one-piece format 2 file.
    pub fn of_file(bytes: &[u8]) -> Result<Bands> {
        let mut rd = ChunkReader::new(bytes, bytes.len() as u64)?;
        let head = match rd.next_chunk()? {
            Ok(c) if &c.kind == b"HEAD" => c,
            _ => return Err(Error::format("no HEAD chunk first", "an .mra file")),
        };
        let header = Header::parse(&head.payload)?;
        if header.version.major != 2 || header.tile != header.dims {
            return Err(Error::format(
                "a tiled or format 1 file",
                "a one-piece format 2 file",
            ));
        }
        let coding = if header.version.has_chosen_coding() {
            Coding::Chosen
        } else {
            Coding::Narrow
        };
        let pyr = if header.mode == Mode::Lossless {
            lossless::plan(&header.dims, header.levels, header.scheme)
        } else {
            let spec = PyramidSpec {
                scheme: header.scheme,
                boundary: header.boundary,
                levels: header.levels,
                order: Order::NonStandard,
                axes: (0..header.dims.len()).collect(),
            };
            Pyramid::plan(&header.dims, &spec)?
        };
        let subs = pyr.subbands();
        let parents: Vec<Option<usize>> = subs
            .iter()
            .map(|b| {
                (b.level > 0)
                    .then(|| {
                        subs.iter()
                            .position(|p| p.level == b.level + 1 && p.high == b.high)
                    })
                    .flatten()
            })
            .collect();
        let ch = header.channels;
        // bands[j * channels + c]
        let mut bands: Vec<Option<Band>> = (0..subs.len() * ch).map(|_| None).collect();
        while let Ok(chunk) = rd.next_chunk()? {
            if &chunk.kind != b"LEVL" {
                continue;
            }
            let mut cur = Cursor::new(&chunk.payload, "LEVL");
            let level = cur.u16()? as usize;
            for j in (0..subs.len()).filter(|&j| subs[j].level == level) {
                for c in 0..ch {
                    let _ratio = cur.f32()?;
                    let len = cur.varint()? as usize;
                    let stream = cur.take(len)?.to_vec();
                    let dims: Vec<usize> = subs[j].ranges.iter().map(|r| r.len()).collect();
                    let kind = if level == 0 {
                        BandKind::Coarse
                    } else {
                        BandKind::Detail
                    };
                    let parent = parents[j].map(|p| p * ch + c);
                    let q = {
                        let par = parent.and_then(|p| bands[p].as_ref()).map(|b| Parent {
                            data: &b.q,
                            dims: &b.dims,
                        });
                        band::decode(&mut Decoder::new_short(&stream), &dims, kind, par, coding)?
                    };
                    let q32 = q
                        .iter()
                        .map(|&v| {
                            i32::try_from(v)
                                .map_err(|_| Error::format("an index over i32", "i32 indices"))
                        })
                        .collect::<Result<Vec<i32>>>()?;
                    bands[j * ch + c] = Some(Band {
                        level,
                        channel: c,
                        kind,
                        dims,
                        parent,
                        q,
                        q32,
                        stream,
                    });
                }
            }
        }
        let bands = bands
            .into_iter()
            .collect::<Option<Vec<Band>>>()
            .ok_or_else(|| Error::format("a band missing", "every band"))?;
        let positions: usize = header.dims.iter().product();
        let raw_bytes = positions * ch * header.sample_type.size();
        Ok(Bands {
            header,
            coding,
            bands,
            raw_bytes,
        })
    }

    /// The parent of band `i` for `entropy::band`.
    pub fn parent(&self, i: usize) -> Option<Parent<'_>> {
        self.bands[i].parent.map(|p| Parent {
            data: &self.bands[p].q,
            dims: &self.bands[p].dims,
        })
    }

    /// The parent of band `i` for `entropy::block`.
    pub fn parent32(&self, i: usize) -> Option<mra::entropy::block::Parent<'_>> {
        self.bands[i].parent.map(|p| mra::entropy::block::Parent {
            data: &self.bands[p].q32,
            dims: &self.bands[p].dims,
        })
    }

    /// Today's coding of band `i` in the classes its stream chose: the same bytes as
    /// the file's stream.
    pub fn encode_today(&self, i: usize) -> Vec<u8> {
        let b = &self.bands[i];
        let wide = self.coding == Coding::Chosen && Decoder::new_short(&b.stream).raw();
        let mut e = Encoder::new();
        if self.coding == Coding::Chosen {
            e.raw(wide);
        }
        let classes = if wide { Classes::Wide } else { Classes::Narrow };
        band::encode(&mut e, &b.q, &b.dims, b.kind, self.parent(i), classes);
        e.finish_short()
    }

    /// Today's decoding of band `i` from `stream`.
    pub fn decode_today(&self, i: usize, stream: &[u8]) -> Result<Vec<i64>> {
        let b = &self.bands[i];
        band::decode(
            &mut Decoder::new_short(stream),
            &b.dims,
            b.kind,
            self.parent(i),
            self.coding,
        )
    }
}
