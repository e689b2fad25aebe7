//! The structured mode: the mutated bytes get every chunk's CRC-32C recomputed before
//! they reach the decoder (the chunks of a `TILE`'s one-tile file too), so a mutation
//! inside a payload is not stopped by its checksum and the container's own checks
//! (order, counts, header fields, lengths, budgets) must reject what is inconsistent.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

/// Offset of the first chunk after the 8-byte signature.
const SIGNATURE_LEN: usize = 8;

/// Rewrite, in place, the CRC of every whole chunk framed in `b[at..]`: the CRC-32C of
/// its type and payload. A `TILE` payload holding chunks (form 0, or a 2.1 tile: the
/// tile index, then form byte 0 in 2.2 and later) has them fixed first. Stops at the first
/// chunk that does not fit.
fn fix_crcs(b: &mut [u8], mut at: usize) {
    while at + 12 <= b.len() {
        let n = u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
        let Some(end) = (at + 12).checked_add(n).filter(|&e| e <= b.len()) else {
            return;
        };
        let body = at + 8;
        if &b[at + 4..at + 8] == b"TILE" && n > 5 && b[body + 4] != 1 {
            // 2.1: chunks right after the index; 2.2+: after form byte 0 (form 1, a
            // compact tile, holds streams, not chunks)
            let skip = if b[body + 4] == 0 { 5 } else { 4 };
            fix_crcs(&mut b[body + skip..body + n], 0);
        }
        let mut c = mra::format::crc::Crc32c::new();
        c.update(&b[at + 4..at + 8]);
        c.update(&b[body..body + n]);
        let crc = c.finish().to_le_bytes();
        b[end - 4..end].copy_from_slice(&crc);
        at = end;
    }
}

fuzz_target!(|data: &[u8]| {
    let mut b = data.to_vec();
    if b.len() > SIGNATURE_LEN {
        fix_crcs(&mut b, SIGNATURE_LEN);
    }
    common::exercise(&b);
});
