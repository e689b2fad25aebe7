//! The chunk types a `.mra` file may hold (formats/MRA.md §2 and the sections of each
//! chunk). A type whose first letter is uppercase is critical (a reader that does not
//! know it refuses the file); lowercase, ancillary (skipped).

/// A chunk type this crate writes or reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Tag {
    /// What the data is and how it was coded (first chunk).
    Head,
    /// The raster's metadata as `key=value` lines (ancillary).
    Meta,
    /// Format 2: the bands of one level, every channel.
    Levl,
    /// Format 1: one band of one channel.
    Band,
    /// Mode 2: the residual layer of one channel.
    Resi,
    /// Tiled files: the step ratios of each tile class (2.2).
    Trat,
    /// Tiled files: the byte offset and length of every `TILE` chunk.
    Tidx,
    /// Tiled files: one tile.
    Tile,
    /// The end of the file (empty payload).
    Mend,
}

impl Tag {
    /// Every tag, in the order of the spec's table.
    pub const ALL: [Tag; 9] = [
        Tag::Head,
        Tag::Meta,
        Tag::Levl,
        Tag::Band,
        Tag::Resi,
        Tag::Trat,
        Tag::Tidx,
        Tag::Tile,
        Tag::Mend,
    ];

    /// The four bytes of the chunk type.
    pub const fn bytes(self) -> &'static [u8; 4] {
        match self {
            Tag::Head => b"HEAD",
            Tag::Meta => b"mETA",
            Tag::Levl => b"LEVL",
            Tag::Band => b"BAND",
            Tag::Resi => b"RESI",
            Tag::Trat => b"TRAT",
            Tag::Tidx => b"TIDX",
            Tag::Tile => b"TILE",
            Tag::Mend => b"MEND",
        }
    }

    /// The chunk type as text.
    pub fn name(self) -> &'static str {
        std::str::from_utf8(self.bytes()).expect("chunk types are ASCII")
    }

    /// The tag of a chunk type, `None` for a type this crate does not know.
    pub fn of(kind: &[u8; 4]) -> Option<Tag> {
        Tag::ALL.into_iter().find(|t| t.bytes() == kind)
    }

    /// Whether a chunk of type `kind` is critical: a reader that does not know it must
    /// refuse the file.
    pub fn is_critical(kind: &[u8; 4]) -> bool {
        kind[0].is_ascii_uppercase()
    }
}

pub const HEAD: &[u8; 4] = Tag::Head.bytes();
pub const META: &[u8; 4] = Tag::Meta.bytes();
pub const LEVL: &[u8; 4] = Tag::Levl.bytes();
pub const BAND: &[u8; 4] = Tag::Band.bytes();
pub const RESI: &[u8; 4] = Tag::Resi.bytes();
pub const TRAT: &[u8; 4] = Tag::Trat.bytes();
pub const TIDX: &[u8; 4] = Tag::Tidx.bytes();
pub const TILE: &[u8; 4] = Tag::Tile.bytes();
pub const MEND: &[u8; 4] = Tag::Mend.bytes();
