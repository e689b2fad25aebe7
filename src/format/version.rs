//! The format version of a file (`HEAD`'s first two bytes) and every rule that depends
//! on it: which versions a reader decodes, which chunks and codings each one has, and
//! which version the writer gives a file (formats/MRA.md §3). The codec asks a
//! [`Version`]; no other module compares version numbers.

use crate::{FormatError, Result};
use std::fmt;

/// A format version `major.minor`. Minor versions of one major add to it: a reader of
/// `2.m` decodes every `2.k` with `k ≤ m` and refuses `2.k` with `k > m` (a 2.3 band
/// would decode wrongly as a 2.2 one).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Version {
    pub major: u8,
    pub minor: u8,
}

impl Version {
    /// Format 1: one `BAND` chunk per band and channel, the adaptive coefficient coding
    /// of [`crate::entropy::v1`] (read only).
    pub const V1: Version = Version::new(1, 0);
    /// 2.0: one `LEVL` chunk per level, the format-2 coefficient coding with narrow
    /// magnitude classes.
    pub const V2_0: Version = Version::new(2, 0);
    /// 2.1: the raster split into tiles (`TIDX` and `TILE` chunks).
    pub const TILED: Version = Version::new(2, 1);
    /// 2.2: a lossy tiled file whose tiles may be compact (a `TRAT` chunk of step ratios
    /// per tile class, a form byte in each `TILE`).
    pub const COMPACT_TILES: Version = Version::new(2, 2);
    /// 2.3: every band's stream chooses its magnitude classes, narrow or wide.
    pub const CHOSEN_CODING: Version = Version::new(2, 3);
    /// 2.4: `HEAD` ends with a flags byte whose bit 0 says the `mETA` lists void samples
    /// (so that a file whose ancillary `mETA` was dropped is refused rather than decoding
    /// its voids as values).
    pub const HEAD_FLAGS: Version = Version::new(2, 4);
    /// 3.0: every band of a one-piece file cut into independent code-blocks, each
    /// `LEVL` band entry an index of block lengths and the blocks (§15); the chosen
    /// coding of 2.3 and the flags byte of 2.4. Tiled files stay 2.x.
    pub const BLOCKS: Version = Version::new(3, 0);
    /// 3.1: 3.0 with a coder byte at the end of `HEAD`: which block coder codes every
    /// code-block of the file (§15.1; 3.0 is coder 0).
    pub const CODER_CHOICE: Version = Version::new(3, 1);
    /// 3.2: the code-block extents shrink with coarser levels by the rule of §15.3
    /// ([`crate::format::Header::block_extents_at`]): no new bytes, `HEAD`'s exponents
    /// are the finest level's; and the coder byte may also name coder 2, the adaptive
    /// quad coder (§15.4).
    pub const LEVEL_BLOCKS: Version = Version::new(3, 2);
    /// The version that brought coder 2: [`Version::LEVEL_BLOCKS`] (3.2 brought both).
    pub const ADAPTIVE_CODER: Version = Version::LEVEL_BLOCKS;
    /// The latest version this reader implements: it refuses later minors of its major.
    pub const LATEST: Version = Version::LEVEL_BLOCKS;
    /// The latest minor of format 2 this reader implements.
    pub const LATEST_2: Version = Version::HEAD_FLAGS;
    /// Every version this reader decodes, oldest first.
    pub const ALL: [Version; 9] = [
        Version::V1,
        Version::V2_0,
        Version::TILED,
        Version::COMPACT_TILES,
        Version::CHOSEN_CODING,
        Version::HEAD_FLAGS,
        Version::BLOCKS,
        Version::CODER_CHOICE,
        Version::LEVEL_BLOCKS,
    ];
    /// The oldest major version readers still decode.
    pub const OLDEST_MAJOR: u8 = 1;

    pub const fn new(major: u8, minor: u8) -> Version {
        Version { major, minor }
    }

    /// `Ok` when a reader of [`Version::LATEST`] decodes files of this version; else an
    /// unsupported-version error naming the versions it reads.
    pub fn check(self) -> Result<Version> {
        let (major, minor) = (self.major, self.minor);
        let (latest, oldest) = (Version::LATEST, Version::OLDEST_MAJOR);
        if !(oldest..=latest.major).contains(&major) {
            return Err(FormatError::Version {
                major,
                minor,
                reads: format!("this reader implements {oldest}.x to {}.x", latest.major),
            }
            .into());
        }
        let top = if major == 2 {
            Version::LATEST_2
        } else {
            latest
        };
        if major >= 2 && major == top.major && minor > top.minor {
            return Err(FormatError::Version {
                major,
                minor,
                reads: format!("this reader implements {}.0 to {top}", top.major),
            }
            .into());
        }
        Ok(self)
    }

    /// Whether this is a format 2 version of minor `v.minor` or later, or format 3
    /// (which keeps every format 2 capability it lists as its own).
    fn at_least(self, v: Version) -> bool {
        (self.major == v.major && self.minor >= v.minor) || self.major == 3
    }

    /// Whether the bands come in `LEVL` chunks (one per level) coded by the format-2
    /// coefficient coding (major 2); else in format 1's `BAND` chunks.
    pub fn has_levels(self) -> bool {
        self.major >= 2
    }

    /// Whether `HEAD` may declare tiles smaller than the raster (2.1 to 2.x; not 3).
    pub fn has_tiles(self) -> bool {
        self.major == 2 && self.at_least(Version::TILED)
    }

    /// Whether a tiled file may hold a `TRAT` chunk and compact `TILE` payloads, each
    /// `TILE` payload starting with its form byte (2.2 to 2.x; not 3).
    pub fn has_compact_tiles(self) -> bool {
        self.major == 2 && self.at_least(Version::COMPACT_TILES)
    }

    /// Whether each band entry of a `LEVL` chunk is a code-block index and its blocks
    /// (3.0, formats/MRA.md §15); else one stream per band.
    pub fn has_blocks(self) -> bool {
        self.major == 3
    }

    /// Whether every band's stream (every code-block's in 3.0) chooses its magnitude
    /// classes (2.3 and later); else the classes are the narrow ones.
    pub fn has_chosen_coding(self) -> bool {
        self.at_least(Version::CHOSEN_CODING)
    }

    /// Whether `HEAD` ends, after the code-block exponents, with the coder byte that
    /// names the block coder of every code-block (3.1 and later 3.x); else coder 0.
    pub fn has_coder_choice(self) -> bool {
        self.major == 3 && self.minor >= 1
    }

    /// Whether the code-block extents shrink with coarser levels (3.2 and later 3.x,
    /// §15.3, [`crate::format::Header::block_extents_at`]); else every band has
    /// `HEAD`'s extents.
    pub fn has_level_blocks(self) -> bool {
        self.major == 3 && self.minor >= 2
    }

    /// Whether the coder byte of a file of this version may name block coder `id`: 0
    /// always, 1 from 3.1, 2 from 3.2; no other id.
    pub fn has_coder(self, id: u8) -> bool {
        match id {
            0 => true,
            1 => self.has_coder_choice(),
            2 => self.has_level_blocks(),
            _ => false,
        }
    }

    /// Whether `HEAD` ends with the flags byte (2.4 and later, 3.0).
    pub fn has_head_flags(self) -> bool {
        self.at_least(Version::HEAD_FLAGS)
    }

    /// The version of a code-block file of version `self` whose blocks are coded by
    /// coder `coder`: `self` for coder 0, at least 3.1 for coder 1 and 3.2 for coder 2
    /// (the oldest that has it). Versions without code-blocks are returned as they are.
    pub fn with_coder(self, coder: u8) -> Version {
        if !self.has_blocks() || coder == 0 {
            self
        } else if coder == 1 {
            self.max(Version::CODER_CHOICE)
        } else {
            self.max(Version::ADAPTIVE_CODER)
        }
    }

    /// The version the writer gives a one-piece file: 3.2 when cut into code-blocks
    /// (`blocks`: blocks that shrink with coarser levels); else 2.3 when lossless (each band chooses its classes), 2.0 when
    /// lossy, 2.4 at least when the `HEAD` says the file has voids. (The one-tile files
    /// inside a tiled file are never cut into code-blocks.)
    pub fn for_file(lossless: bool, voids: bool, blocks: bool) -> Version {
        if blocks {
            return Version::LEVEL_BLOCKS;
        }
        let v = if lossless {
            Version::CHOSEN_CODING
        } else {
            Version::V2_0
        };
        if voids {
            v.max(Version::HEAD_FLAGS)
        } else {
            v
        }
    }

    /// The version of a tiled file's `HEAD` (its tiles' one-tile files keep their own):
    /// 2.2 when lossy (compact tiles), 2.1 else.
    pub fn for_tiled(lossy: bool) -> Version {
        if lossy {
            Version::COMPACT_TILES
        } else {
            Version::TILED
        }
    }

    /// The version of the one-tile file a compact tile stands for (2.0: narrow classes,
    /// no flags byte).
    pub fn of_compact_tile() -> Version {
        Version::V2_0
    }
}

impl fmt::Display for Version {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.major, self.minor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capabilities_follow_the_minor_versions() {
        for v in Version::ALL {
            assert!(v.check().is_ok(), "{v}");
            let three = v.major == 3;
            assert_eq!(v.has_levels(), v.major >= 2);
            assert_eq!(v.has_tiles(), v.major == 2 && v.minor >= 1, "{v}");
            assert_eq!(v.has_compact_tiles(), v.major == 2 && v.minor >= 2, "{v}");
            let two = |m| v.major == 2 && v.minor >= m;
            assert_eq!(v.has_chosen_coding(), two(3) || three, "{v}");
            assert_eq!(v.has_head_flags(), two(4) || three, "{v}");
            assert_eq!(v.has_blocks(), three, "{v}");
            assert_eq!(v.has_coder_choice(), three && v.minor >= 1, "{v}");
            assert_eq!(v.has_level_blocks(), three && v.minor >= 2, "{v}");
        }
        // format 1 has none of format 2's minors, whatever its minor byte
        assert!(!Version::new(1, 9).has_tiles() && !Version::new(1, 9).has_head_flags());
        assert!(Version::new(2, Version::LATEST_2.minor + 1)
            .check()
            .is_err());
        assert!(Version::new(3, 3).check().is_err() && Version::new(4, 0).check().is_err());
        assert_eq!(Version::LEVEL_BLOCKS.with_coder(1), Version::LEVEL_BLOCKS);
        assert_eq!(Version::BLOCKS.with_coder(0), Version::BLOCKS);
        assert_eq!(Version::BLOCKS.with_coder(1), Version::CODER_CHOICE);
        assert_eq!(Version::BLOCKS.with_coder(2), Version::ADAPTIVE_CODER);
        assert_eq!(
            Version::ADAPTIVE_CODER.with_coder(1),
            Version::ADAPTIVE_CODER
        );
        for v in Version::ALL {
            assert!(v.has_coder(0) && !v.has_coder(3), "{v}");
            assert_eq!(v.has_coder(1), v >= Version::CODER_CHOICE, "{v}");
            assert_eq!(v.has_coder(2), v >= Version::ADAPTIVE_CODER, "{v}");
        }
        assert_eq!(Version::HEAD_FLAGS.with_coder(1), Version::HEAD_FLAGS);
        assert!(Version::new(0, 0).check().is_err());
    }
}
